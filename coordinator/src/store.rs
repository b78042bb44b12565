//! The results store: one SQLite database (WAL mode) per results directory, one row per job.
//! A row is committed before its result is acknowledged, so a killed coordinator loses nothing
//! it acknowledged, and a second run skips every stored job.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use rusqlite::{params, Connection, OptionalExtension};

use floorcast_worker::tour::TourRecord;
pub use floorcast_worker::wire::JobStatus;
use floorcast_worker::{RunSummary, Settings};

pub use floorcast_stats::StoredResult;

/// Version of the database layout.
pub const STORE_VERSION: u32 = 1;
pub const DB_FILE: &str = "results.sqlite";
/// The lock a `floorcast run` holds on its results directory while it runs.
pub const LOCK_FILE: &str = "floorcast.lock";
/// Every file floorcast owns in a results directory: the store, SQLite's files beside it and the
/// run's lock. No export may write to one of them.
pub const OWNED_FILES: [&str; 5] = [
    DB_FILE,
    "results.sqlite-wal",
    "results.sqlite-shm",
    "results.sqlite-journal",
    LOCK_FILE,
];

#[derive(Debug, thiserror::Error)]
pub enum StoreError {
    #[error("results store {path}: {source}")]
    Sql {
        path: PathBuf,
        source: rusqlite::Error,
    },
    #[error("cannot create results directory {path}: {source}")]
    Dir {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("results store {path} has layout version {found}, this floorcast writes version {STORE_VERSION}; use another --results directory")]
    Version { path: PathBuf, found: String },
    #[error("no results store in {0} (expected {DB_FILE}); run `floorcast run GRID` first")]
    Missing(PathBuf),
    #[error("{path} is not a floorcast results store ({why}); floorcast leaves it untouched: give another --results directory")]
    Foreign { path: PathBuf, why: String },
    #[error("results store {path} is damaged ({why}); floorcast leaves it untouched: restore it from a copy, salvage its rows with `sqlite3 {path} .recover`, or give another --results directory")]
    Damaged { path: PathBuf, why: String },
    #[error("results store {path} is locked by another program ({why}); end the program holding it (an sqlite3 shell, a backup) and try again")]
    Busy { path: PathBuf, why: String },
    #[error("results store {path} is read-only ({why}); `floorcast run` writes it: make it and its folder writable or give another --results directory (`floorcast report` reads it as it is)")]
    ReadOnly { path: PathBuf, why: String },
    #[error("results store {path} cannot be read ({why}); give yourself read access to it, or give another --results directory")]
    Unreadable { path: PathBuf, why: String },
    #[error("results store {path} was created by floorcast but never finished (it holds no results, no store version: its disk was full, or floorcast was killed as it made it); `floorcast run GRID --results {dir}` completes it")]
    HalfMade { path: PathBuf, dir: PathBuf },
    #[error("results store {path}: {problem}")]
    Row { path: PathBuf, problem: String },
    #[error("results directory {dir} is in use by another floorcast run ({holder}); wait for it to end or stop it, then run again (report needs no lock)")]
    Locked { dir: PathBuf, holder: String },
    #[error("cannot lock {path} ({source}); give a --results directory you can write")]
    Lock {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("the lock {path} is {what}; floorcast writes its lock only to a file of its own: remove it (nothing runs while it is there) and run again")]
    LockNotOwn { path: PathBuf, what: String },
    #[error("{flag}: {path} is {owned}, a file floorcast owns; writing there would destroy the results: give another path")]
    Owned {
        flag: String,
        path: PathBuf,
        owned: PathBuf,
    },
}

/// One failed attempt of a job, as the `failures` table keeps it: every failure is recorded
/// when it is stored (first attempts included), and kept when the job is run again
/// (`run --retry-failed`), whatever the new attempt gives.
#[derive(Debug, Clone, PartialEq)]
pub struct Failure {
    pub job_id: String,
    /// 1 for the job's first failure, then 2, 3...
    pub attempt: u32,
    pub grid: String,
    pub building: String,
    pub strategy: String,
    pub label: String,
    pub seed: u64,
    pub error: String,
    /// The end of the strategy program's stderr, if it had one.
    pub stderr_tail: Option<String>,
    pub worker: String,
    pub wall_time_s: f64,
    pub floorcast_version: String,
    pub stored_unix_s: f64,
}

/// What the running floorcast was built from: its own commit (not the current directory's),
/// whether its code differed from that commit, and the build profile. The binary embeds them
/// at build time (its `build.rs`) and hands them to [`provenance`].
#[derive(Debug, Clone, PartialEq)]
pub struct BuildInfo {
    /// floorcast's commit (40 hex digits), or "unknown" when not built from a git checkout.
    pub git_commit: String,
    pub git_dirty: bool,
    /// "release" or "debug".
    pub profile: String,
}

/// Where a grid run came from.
#[derive(Debug, Clone, PartialEq)]
pub struct Provenance {
    pub grid: String,
    pub command: String,
    /// floorcast's own commit and dirty flag ([`BuildInfo`]).
    pub git_commit: String,
    pub git_dirty: bool,
    pub build_profile: String,
    /// The commit of the repository of the directory `run` ran in (the user's experiments,
    /// say), "none" outside one.
    pub cwd_git_commit: String,
    pub cwd_git_dirty: bool,
    pub rustc: String,
    pub host: String,
    pub floorcast_version: String,
    pub started_unix_s: f64,
}

#[derive(Debug)]
pub struct Store {
    path: PathBuf,
    conn: Connection,
    /// Opened by [`Store::open`] as a store floorcast had created but not finished
    /// ([`StoreError::HalfMade`]), now completed.
    completed: bool,
    /// The tables and columns added since the first layout are there ([`Store::upgrade`]).
    upgraded: std::sync::atomic::AtomicBool,
}

impl Store {
    /// Opens (creating if needed) the store in `dir` to write it (`run`). A file already there
    /// is checked first ([`check_is_store`]) without writing anything.
    pub fn open(dir: &Path) -> Result<Store, StoreError> {
        std::fs::create_dir_all(dir).map_err(|source| StoreError::Dir {
            path: dir.to_path_buf(),
            source,
        })?;
        let path = dir.join(DB_FILE);
        let mut completed = false;
        if std::fs::symlink_metadata(&path).is_ok() {
            match check_is_store(&path) {
                Ok(_) => {}
                // It holds nothing: made whole below, as a new store is.
                Err(StoreError::HalfMade { .. }) => completed = true,
                Err(e) => return Err(e),
            }
            // Refused before SQLite opens it (and makes its files beside it) read-only.
            if let Err(e) = std::fs::OpenOptions::new().write(true).open(&path) {
                return Err(StoreError::ReadOnly {
                    path,
                    why: e.to_string(),
                });
            }
        }
        let conn = Connection::open(&path).map_err(|e| classify(&path, e))?;
        let s = Store {
            path,
            conn,
            completed,
            upgraded: false.into(),
        };
        s.init()?;
        Ok(s)
    }

    /// Opens the store in `dir` to read it (`report`, `run --summary`): checked first, never
    /// written, and nothing created beside it; errors if absent.
    pub fn open_existing(dir: &Path) -> Result<Store, StoreError> {
        let path = dir.join(DB_FILE);
        if !dir.is_dir() || std::fs::symlink_metadata(&path).is_err() {
            return Err(StoreError::Missing(dir.to_path_buf()));
        }
        let conn = check_is_store(&path)?;
        Ok(Store {
            path,
            conn,
            completed: false,
            upgraded: false.into(),
        })
    }

    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Whether [`Store::open`] found a store floorcast had created but not finished (it held
    /// nothing) and completed it.
    pub fn completed_half_made(&self) -> bool {
        self.completed
    }
}

/// A results directory's lock ([`LOCK_FILE`]), held by one `floorcast run` for as long as it
/// runs: the system releases it when the process ends, however it ends. The file says who holds
/// it (process id and host).
#[derive(Debug)]
pub struct RunLock {
    _file: std::fs::File,
}

/// Takes `dir`'s lock (creating the directory), or refuses at once if another process holds
/// it, naming it. Reading a store (`report`) needs no lock.
pub fn lock_results(dir: &Path) -> Result<RunLock, StoreError> {
    use std::io::{Read, Seek, Write};
    std::fs::create_dir_all(dir).map_err(|source| StoreError::Dir {
        path: dir.to_path_buf(),
        source,
    })?;
    let path = dir.join(LOCK_FILE);
    let failed = |source: std::io::Error| match source.kind() {
        std::io::ErrorKind::PermissionDenied | std::io::ErrorKind::ReadOnlyFilesystem => {
            StoreError::ReadOnly {
                path: dir.join(DB_FILE),
                why: format!("its folder cannot be written: {source}"),
            }
        }
        _ => StoreError::Lock {
            path: path.clone(),
            source,
        },
    };
    // The lock is a file of floorcast's own: a symbolic link there is refused, never followed
    // (its target would be written), and so is anything but a regular file.
    let not_own = |what: &str| StoreError::LockNotOwn {
        path: path.clone(),
        what: what.to_string(),
    };
    if let Ok(m) = std::fs::symlink_metadata(&path) {
        if m.file_type().is_symlink() {
            return Err(not_own("a symbolic link"));
        }
        if !m.is_file() {
            return Err(not_own("not a regular file"));
        }
    }
    let mut file = std::fs::OpenOptions::new()
        .read(true)
        .write(true)
        .create(true)
        .truncate(false)
        .open(&path)
        .map_err(failed)?;
    {
        // What was opened is what is there now (not a link put in its place meanwhile).
        use std::os::unix::fs::MetadataExt;
        let opened = file.metadata().map_err(failed)?;
        match std::fs::symlink_metadata(&path) {
            Ok(m) if m.is_file() && m.dev() == opened.dev() && m.ino() == opened.ino() => {}
            _ => return Err(not_own("replaced while it was opened")),
        }
    }
    match file.try_lock() {
        Ok(()) => {}
        Err(std::fs::TryLockError::WouldBlock) => {
            let mut text = String::new();
            let _ = file.take(4096).read_to_string(&mut text);
            let holder: String = text
                .trim()
                .chars()
                .map(|c| if c.is_control() { ' ' } else { c })
                .take(200)
                .collect();
            return Err(StoreError::Locked {
                dir: dir.to_path_buf(),
                holder: if holder.is_empty() {
                    "its process id unknown".into()
                } else {
                    holder
                },
            });
        }
        Err(std::fs::TryLockError::Error(e)) => return Err(failed(e)),
    }
    file.set_len(0)
        .and_then(|_| file.rewind())
        .and_then(|_| writeln!(file, "pid {} on host {}", std::process::id(), host_name()))
        .map_err(failed)?;
    Ok(RunLock { _file: file })
}

/// Refuses an output path (`report --csv`, `--json`, `--html`) that is one of the files
/// floorcast owns in `results_dir` ([`OWNED_FILES`]), whatever its spelling: relative, with
/// `.` or `..`, through symbolic links, or a hard link (the same device and inode). `None` (the
/// flag not given) passes. Nothing is written.
pub fn refuse_owned(flag: &str, out: Option<&Path>, results_dir: &Path) -> Result<(), StoreError> {
    let Some(out) = out else { return Ok(()) };
    match owned_file_at(out, results_dir) {
        Some(owned) => Err(StoreError::Owned {
            flag: flag.to_string(),
            path: out.to_path_buf(),
            owned,
        }),
        None => Ok(()),
    }
}

/// [`refuse_owned`] for a directory of charts (`report --plots`): every file there with the
/// charts' extension `ext` (one a chart may overwrite), a symbolic link included, is checked.
pub fn refuse_owned_in(
    flag: &str,
    dir: Option<&Path>,
    ext: &str,
    results_dir: &Path,
) -> Result<(), StoreError> {
    let Some(dir) = dir else { return Ok(()) };
    refuse_owned(flag, Some(dir), results_dir)?;
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Ok(());
    };
    for e in entries.flatten() {
        let path = e.path();
        if path.extension().and_then(|x| x.to_str()) == Some(ext) {
            refuse_owned(flag, Some(&path), results_dir)?;
        }
    }
    Ok(())
}

/// The file of [`OWNED_FILES`] in `results_dir` that writing `out` would write, if any.
fn owned_file_at(out: &Path, results_dir: &Path) -> Option<PathBuf> {
    OWNED_FILES
        .iter()
        .map(|f| results_dir.join(f))
        .find(|owned| same_file(out, owned))
}

/// Whether writing `a` would write `b`, whatever their spellings: relative, with `.` or `..`,
/// through symbolic links (a link to a file not yet there included), or a hard link (both
/// there: the same device and inode).
pub fn same_file(a: &Path, b: &Path) -> bool {
    use std::os::unix::fs::MetadataExt;
    match (std::fs::metadata(a), std::fs::metadata(b)) {
        (Ok(x), Ok(y)) => x.dev() == y.dev() && x.ino() == y.ino(),
        _ => {
            let ra = resolved(a);
            ra.is_some() && ra == resolved(b)
        }
    }
}

/// Where writing `path` would write: its absolute path with every symbolic link followed, a
/// link to a file not yet there included (`None` when its directory does not exist, or it has
/// no file name).
pub fn resolved(path: &Path) -> Option<PathBuf> {
    let mut p = std::path::absolute(path).ok()?;
    // As many links as the kernel follows.
    for _ in 0..40 {
        if let Ok(c) = p.canonicalize() {
            return Some(c);
        }
        let name = p.file_name()?.to_owned();
        let full = p.parent()?.canonicalize().ok()?.join(name);
        match std::fs::read_link(&full) {
            Ok(target) => p = full.parent()?.join(target),
            Err(_) => return Some(full),
        }
    }
    None
}

/// SQLite's header: the first 16 bytes of every SQLite database file.
const SQLITE_HEADER: &[u8; 16] = b"SQLite format 3\0";

/// How long a store another program holds locked is waited for.
const BUSY_WAIT: std::time::Duration = std::time::Duration::from_secs(5);

/// Opens `path` read-only, creating no file beside it, and checks it is a whole floorcast store:
/// refuses, without writing anything, a file that is not one (foreign: not a file, not SQLite, a
/// database without floorcast's store version), a damaged one (empty, truncated, failing
/// `PRAGMA integrity_check`, its results table missing), one locked by another program, and one
/// that cannot be read; each with its own message. Returns the read-only connection.
///
/// A store whose write-ahead log (`-wal`) is absent is whole in its one file (SQLite merges the
/// log when its last connection closes), and is read as immutable: nothing is created, so a
/// store in a folder one cannot write is read too. With a log present (a run writing it, or one
/// that was killed), it is opened read-only through SQLite's locks.
fn check_is_store(path: &Path) -> Result<Connection, StoreError> {
    check_sqlite_file(path)?;
    let wal = PathBuf::from(format!("{}-wal", path.display()));
    let logged = std::fs::symlink_metadata(&wal).is_ok();
    let conn = Connection::open_with_flags(
        sqlite_uri(path, if logged { "mode=ro" } else { "immutable=1" }),
        rusqlite::OpenFlags::SQLITE_OPEN_READ_ONLY
            | rusqlite::OpenFlags::SQLITE_OPEN_NO_MUTEX
            | rusqlite::OpenFlags::SQLITE_OPEN_URI,
    )
    .map_err(|e| classify(path, e))?;
    conn.busy_timeout(BUSY_WAIT)
        .map_err(|e| classify(path, e))?;
    let tables: Vec<String> = conn
        .prepare("SELECT name FROM sqlite_master WHERE type = 'table'")
        .and_then(|mut st| {
            st.query_map([], |r| r.get::<_, String>(0))?
                .collect::<Result<Vec<_>, _>>()
        })
        .map_err(|e| match classify(path, e) {
            StoreError::ReadOnly { why, .. } if logged => StoreError::ReadOnly {
                path: path.to_path_buf(),
                why: format!(
                    "{why}; its write-ahead log {} holds rows SQLite must merge, which needs \
                     a folder it can write: copy the folder somewhere writable and read the copy",
                    wal.display()
                ),
            },
            e => e,
        })?;
    check_floorcast_tables(&conn, &tables, path)?;
    Ok(conn)
}

/// The store at `path` is another program's file.
fn foreign(path: &Path, why: &str) -> StoreError {
    StoreError::Foreign {
        path: path.to_path_buf(),
        why: why.to_string(),
    }
}

/// The store at `path` is damaged.
fn damaged(path: &Path, why: &str) -> StoreError {
    StoreError::Damaged {
        path: path.to_path_buf(),
        why: why.to_string(),
    }
}

/// The file at `path` is a regular, non-empty file starting with SQLite's header.
fn check_sqlite_file(path: &Path) -> Result<(), StoreError> {
    let meta = std::fs::metadata(path).map_err(|e| StoreError::Unreadable {
        path: path.to_path_buf(),
        why: e.to_string(),
    })?;
    if !meta.is_file() {
        return Err(foreign(path, "not a regular file"));
    }
    if meta.len() == 0 {
        if ran_in(path) {
            return Err(half_made(path));
        }
        return Err(damaged(path, "an empty file"));
    }
    let mut header = [0u8; 16];
    {
        use std::io::Read;
        let mut f = std::fs::File::open(path).map_err(|e| StoreError::Unreadable {
            path: path.to_path_buf(),
            why: e.to_string(),
        })?;
        let n = f.read(&mut header).map_err(|e| StoreError::Unreadable {
            path: path.to_path_buf(),
            why: e.to_string(),
        })?;
        if n < header.len() || &header != SQLITE_HEADER {
            // A folder a run has used holds its lock: the store there was damaged at its start.
            let used = path
                .parent()
                .is_some_and(|d| std::fs::symlink_metadata(d.join(LOCK_FILE)).is_ok());
            return Err(if used {
                damaged(
                    path,
                    "its first bytes are not SQLite's header, in a folder floorcast has run in",
                )
            } else {
                foreign(path, "not an SQLite database: a store damaged at its start, or another program's file")
            });
        }
    }
    Ok(())
}

/// Whether a `floorcast run` has used the folder of the store at `path` (its lock is there).
fn ran_in(path: &Path) -> bool {
    path.parent()
        .is_some_and(|d| std::fs::symlink_metadata(d.join(LOCK_FILE)).is_ok())
}

fn half_made(path: &Path) -> StoreError {
    StoreError::HalfMade {
        path: path.to_path_buf(),
        dir: path.parent().unwrap_or(Path::new(".")).to_path_buf(),
    }
}

/// Whether the SQLite file at `path` is in write-ahead-log mode (its header's bytes 18 and 19).
fn wal_mode(path: &Path) -> bool {
    use std::io::Read;
    let mut header = [0u8; 20];
    std::fs::File::open(path)
        .and_then(|mut f| f.read_exact(&mut header))
        .is_ok_and(|()| header[18] == 2 && header[19] == 2)
}

/// The tables a floorcast store may hold (SQLite's own `sqlite_sequence` included).
const STORE_TABLES: [&str; 8] = [
    "meta",
    "results",
    "runs",
    "sequential",
    "failures",
    "grids",
    "tours",
    "sqlite_sequence",
];

/// Whether the database is a store floorcast began and could not finish: in write-ahead-log
/// mode (what floorcast sets first, [`Store::init`]), it holds none but floorcast's tables (none
/// at all, as a store whose creation failed on a full disk), every one empty, and so no store
/// version either.
fn is_half_made(conn: &Connection, tables: &[String], path: &Path) -> bool {
    wal_mode(path)
        && tables.iter().all(|t| STORE_TABLES.contains(&t.as_str()))
        && tables.iter().all(|t| {
            conn.query_row(
                &format!("SELECT NOT EXISTS (SELECT 1 FROM \"{t}\")"),
                [],
                |r| r.get::<_, bool>(0),
            )
            .unwrap_or(false)
        })
}

/// An SQLite database with `tables` is floorcast's store of this version, whole.
fn check_floorcast_tables(
    conn: &Connection,
    tables: &[String],
    path: &Path,
) -> Result<(), StoreError> {
    if is_half_made(conn, tables, path) {
        return Err(half_made(path));
    }
    if !tables.iter().any(|t| t == "meta") {
        return Err(foreign(
            path,
            "an SQLite database without floorcast's tables",
        ));
    }
    let version: Option<String> = conn
        .query_row(
            "SELECT value FROM meta WHERE key = 'store_version'",
            [],
            |r| r.get(0),
        )
        .optional()
        .map_err(|e| classify(path, e))?;
    match version {
        None => {
            return Err(foreign(
                path,
                "an SQLite database without a floorcast store version",
            ))
        }
        Some(v) if v != STORE_VERSION.to_string() => {
            return Err(StoreError::Version {
                path: path.to_path_buf(),
                found: floorcast_worker::text::excerpt(&v),
            })
        }
        Some(_) => {}
    }
    if !tables.iter().any(|t| t == "results") {
        return Err(damaged(path, "its results table is missing"));
    }
    let problems: Vec<String> = conn
        .prepare("PRAGMA integrity_check(3)")
        .and_then(|mut st| {
            st.query_map([], |r| r.get::<_, String>(0))?
                .collect::<Result<Vec<_>, _>>()
        })
        .map_err(|e| classify(path, e))?;
    if problems != ["ok"] {
        return Err(damaged(
            path,
            &format!(
                "PRAGMA integrity_check: {}",
                floorcast_worker::text::shown(&problems.join("; "), 200)
            ),
        ));
    }
    Ok(())
}

/// SQLite's URI for `path` (every byte but the unreserved ones percent-encoded) with `query`.
fn sqlite_uri(path: &Path, query: &str) -> String {
    use std::os::unix::ffi::OsStrExt;
    let abs = std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf());
    let mut uri = String::from("file:");
    for &b in abs.as_os_str().as_bytes() {
        if b.is_ascii_alphanumeric() || b"/-._~".contains(&b) {
            uri.push(b as char);
        } else {
            uri.push_str(&format!("%{b:02X}"));
        }
    }
    uri.push('?');
    uri.push_str(query);
    uri
}

/// SQLite's error on store `path`, told apart: damaged (corrupt, not a database), locked by
/// another program, read-only, unreadable, or another error.
fn classify(path: &Path, e: rusqlite::Error) -> StoreError {
    use rusqlite::ErrorCode as C;
    let path_buf = path.to_path_buf();
    if let rusqlite::Error::SqliteFailure(f, message) = &e {
        let why = message.clone().unwrap_or_else(|| f.to_string());
        match f.code {
            C::DatabaseCorrupt | C::NotADatabase => {
                return StoreError::Damaged {
                    path: path_buf,
                    why,
                }
            }
            C::DatabaseBusy | C::DatabaseLocked => {
                return StoreError::Busy {
                    path: path_buf,
                    why,
                }
            }
            C::ReadOnly => {
                return StoreError::ReadOnly {
                    path: path_buf,
                    why,
                }
            }
            C::PermissionDenied | C::CannotOpen => {
                // Unreadable, or a folder in which SQLite cannot make its files.
                return match std::fs::File::open(path) {
                    Err(io) => StoreError::Unreadable {
                        path: path_buf,
                        why: io.to_string(),
                    },
                    Ok(_) => StoreError::ReadOnly {
                        path: path_buf,
                        why: format!("{why}: SQLite cannot create its files beside it"),
                    },
                };
            }
            _ => {}
        }
    }
    StoreError::Sql {
        path: path_buf,
        source: e,
    }
}

impl Store {
    fn sql<T>(&self, r: rusqlite::Result<T>) -> Result<T, StoreError> {
        r.map_err(|e| classify(&self.path, e))
    }

    fn init(&self) -> Result<(), StoreError> {
        self.sql(self.conn.pragma_update(None, "journal_mode", "WAL"))?;
        // WAL + NORMAL: a committed transaction survives the process being killed at any moment
        // (what acknowledgements promise); only a power cut can lose the last ones. FULL would
        // add a disk sync per commit (measured: 1.4k -> 0.7k results/s through zenoh).
        self.sql(self.conn.pragma_update(None, "synchronous", "NORMAL"))?;
        self.sql(self.conn.busy_timeout(std::time::Duration::from_secs(10)))?;
        self.sql(self.conn.execute_batch(
            "CREATE TABLE IF NOT EXISTS meta (key TEXT PRIMARY KEY, value TEXT NOT NULL);
             CREATE TABLE IF NOT EXISTS results (
                job_id TEXT PRIMARY KEY,
                grid TEXT NOT NULL,
                building TEXT NOT NULL,
                building_hash TEXT NOT NULL,
                strategy TEXT NOT NULL,
                label TEXT NOT NULL,
                seed INTEGER NOT NULL,
                settings_json TEXT NOT NULL,
                status TEXT NOT NULL,
                error TEXT,
                summary_json TEXT,
                progress_csv TEXT,
                worker TEXT NOT NULL,
                wall_time_s REAL NOT NULL,
                floorcast_version TEXT NOT NULL,
                stored_unix_s REAL NOT NULL
             );
             CREATE TABLE IF NOT EXISTS runs (
                id INTEGER PRIMARY KEY AUTOINCREMENT,
                grid TEXT NOT NULL,
                command TEXT NOT NULL,
                git_commit TEXT NOT NULL,
                git_dirty INTEGER NOT NULL,
                rustc TEXT NOT NULL,
                host TEXT NOT NULL,
                floorcast_version TEXT NOT NULL,
                started_unix_s REAL NOT NULL
             );
             CREATE TABLE IF NOT EXISTS sequential (
                grid TEXT NOT NULL,
                label TEXT NOT NULL,
                reference TEXT NOT NULL,
                through_seed INTEGER NOT NULL,
                pairs INTEGER NOT NULL,
                mean REAL NOT NULL,
                variance REAL NOT NULL,
                llr REAL NOT NULL,
                lower REAL NOT NULL,
                upper REAL NOT NULL,
                decision TEXT NOT NULL,
                PRIMARY KEY (grid, label, reference, through_seed)
             );",
        ))?;
        let found: Option<String> = self.sql(
            self.conn
                .query_row(
                    "SELECT value FROM meta WHERE key = 'store_version'",
                    [],
                    |r| r.get(0),
                )
                .optional(),
        )?;
        match found {
            None => {
                self.sql(self.conn.execute(
                    "INSERT INTO meta (key, value) VALUES ('store_version', ?1)",
                    params![STORE_VERSION.to_string()],
                ))?;
            }
            Some(v) if v == STORE_VERSION.to_string() => {}
            Some(v) => {
                return Err(StoreError::Version {
                    path: self.path.clone(),
                    found: v,
                })
            }
        }
        Ok(())
    }

    /// Adds what a store written by an earlier version lacks: the `failures` table and the
    /// columns of [`ADDED_COLUMNS`] (each nullable: its old rows hold none). Done once, by the
    /// first write (as `grids` and `tours` are made): opening a store changes nothing in it,
    /// so that a store refused after it was opened (a tampered row) is left as it was.
    fn upgrade(&self) -> Result<(), StoreError> {
        use std::sync::atomic::Ordering;
        if self.upgraded.load(Ordering::SeqCst) {
            return Ok(());
        }
        self.sql(self.conn.execute_batch(
            "CREATE TABLE IF NOT EXISTS failures (
                job_id TEXT NOT NULL,
                attempt INTEGER NOT NULL,
                grid TEXT NOT NULL,
                building TEXT NOT NULL,
                strategy TEXT NOT NULL,
                label TEXT NOT NULL,
                seed INTEGER NOT NULL,
                error TEXT NOT NULL,
                stderr_tail TEXT,
                worker TEXT NOT NULL,
                wall_time_s REAL NOT NULL,
                floorcast_version TEXT NOT NULL,
                stored_unix_s REAL NOT NULL,
                PRIMARY KEY (job_id, attempt)
             );",
        ))?;
        for (table, column, kind) in ADDED_COLUMNS {
            if !self.has_column(table, column)? {
                self.sql(
                    self.conn
                        .execute_batch(&format!("ALTER TABLE {table} ADD COLUMN {column} {kind};")),
                )?;
            }
        }
        self.upgraded.store(true, Ordering::SeqCst);
        Ok(())
    }

    /// Whether `table` has `column` (stores of earlier builds lack the newer ones).
    fn has_column(&self, table: &str, column: &str) -> Result<bool, StoreError> {
        let n: i64 = self.sql(self.conn.query_row(
            "SELECT count(*) FROM pragma_table_info(?1) WHERE name = ?2",
            [table, column],
            |r| r.get(0),
        ))?;
        Ok(n > 0)
    }

    /// Stores a result unless one for the same job exists. Returns whether it was inserted.
    /// The row is committed (durable) when this returns.
    pub fn insert(&self, r: &StoredResult) -> Result<bool, StoreError> {
        Ok(self.insert_many(std::slice::from_ref(r))? == 1)
    }

    /// Stores results (skipping jobs already stored) in one transaction, so that a burst of
    /// results costs one disk sync. Every failure stored is also recorded in the `failures`
    /// table, with its attempt number. Every row is committed when this returns; returns how
    /// many were stored.
    pub fn insert_many(&self, rows: &[StoredResult]) -> Result<usize, StoreError> {
        self.insert_many_replacing(rows, &BTreeSet::new())
    }

    /// [`Store::insert_many`], where a row of a job in `retried` (a job run again by `run
    /// --retry-failed`) replaces the job's failed row; the failure it replaces stays in the
    /// `failures` table.
    pub fn insert_many_replacing(
        &self,
        rows: &[StoredResult],
        retried: &BTreeSet<String>,
    ) -> Result<usize, StoreError> {
        if rows.is_empty() {
            return Ok(0);
        }
        self.upgrade()?;
        let now = unix_now_s();
        let tx = self.sql(self.conn.unchecked_transaction())?;
        let mut inserted = 0;
        for r in rows {
            inserted += self.insert_row(&tx, r, now, retried.contains(&r.job_id))?;
        }
        self.sql(tx.commit())?;
        Ok(inserted)
    }

    fn insert_row(
        &self,
        conn: &Connection,
        r: &StoredResult,
        now: f64,
        replace_failed: bool,
    ) -> Result<usize, StoreError> {
        let settings_json = serde_json::to_string(&r.settings).unwrap_or_default();
        let summary_json = r
            .summary
            .as_ref()
            .and_then(|s| serde_json::to_string(s).ok());
        let progress_csv = r.progress.as_deref().map(floorcast_stats::progress::encode);
        // A failed row about to be replaced keeps its place in the history: one written before
        // failures were recorded becomes the job's first attempt.
        if replace_failed {
            self.sql(conn.execute(
            "INSERT INTO failures (job_id, attempt, grid, building, strategy, label, seed, error,
                stderr_tail, worker, wall_time_s, floorcast_version, stored_unix_s)
             SELECT job_id, 1, grid, building, strategy, label, seed, COALESCE(error, ''),
                stderr_tail, worker, wall_time_s, floorcast_version, stored_unix_s
             FROM results WHERE job_id = ?1 AND status = 'failed'
                AND NOT EXISTS (SELECT 1 FROM failures WHERE job_id = ?1)",
                [&r.job_id],
            ))?;
        }
        let stored = self.sql(conn.execute(
            "INSERT INTO results (job_id, grid, building, building_hash, strategy, label, seed,
                settings_json, status, error, summary_json, progress_csv, worker, wall_time_s,
                floorcast_version, stored_unix_s, stderr_tail)
             VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ?11, ?12, ?13, ?14, ?15, ?16, ?17)
             ON CONFLICT(job_id) DO UPDATE SET grid = excluded.grid, building = excluded.building,
                building_hash = excluded.building_hash, strategy = excluded.strategy,
                label = excluded.label, seed = excluded.seed, settings_json = excluded.settings_json,
                status = excluded.status, error = excluded.error,
                summary_json = excluded.summary_json, progress_csv = excluded.progress_csv,
                worker = excluded.worker, wall_time_s = excluded.wall_time_s,
                floorcast_version = excluded.floorcast_version,
                stored_unix_s = excluded.stored_unix_s, stderr_tail = excluded.stderr_tail
             WHERE results.status = 'failed' AND ?18",
            params![
                r.job_id, r.grid, r.building, r.building_hash, r.strategy, r.label, r.seed as i64,
                settings_json, r.status.as_str(), r.error, summary_json, progress_csv, r.worker,
                r.wall_time_s, r.floorcast_version, now, r.stderr_tail, replace_failed
            ],
        ))?;
        if stored == 1 && r.status == JobStatus::Failed {
            self.sql(conn.execute(
                "INSERT INTO failures (job_id, attempt, grid, building, strategy, label, seed,
                    error, stderr_tail, worker, wall_time_s, floorcast_version, stored_unix_s)
                 VALUES (?1, (SELECT COALESCE(MAX(attempt), 0) + 1 FROM failures WHERE job_id = ?1),
                    ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ?11, ?12)",
                params![
                    r.job_id,
                    r.grid,
                    r.building,
                    r.strategy,
                    r.label,
                    r.seed as i64,
                    r.error.as_deref().unwrap_or(""),
                    r.stderr_tail,
                    r.worker,
                    r.wall_time_s,
                    r.floorcast_version,
                    now
                ],
            ))?;
        }
        Ok(stored)
    }

    /// Deletes every row `worker` returned (its results were found wrong) in one transaction
    /// and returns their job ids, so that they run again.
    pub fn discard_worker(&self, worker: &str) -> Result<Vec<String>, StoreError> {
        let tx = self.sql(self.conn.unchecked_transaction())?;
        let ids = {
            let mut st = self.sql(tx.prepare("SELECT job_id FROM results WHERE worker = ?1"))?;
            let rows = self.sql(st.query_map([worker], |r| r.get::<_, String>(0)))?;
            let mut ids = Vec::new();
            for r in rows {
                ids.push(self.sql(r)?);
            }
            ids
        };
        self.sql(tx.execute("DELETE FROM results WHERE worker = ?1", [worker]))?;
        self.sql(tx.commit())?;
        Ok(ids)
    }

    /// Stores `row`, replacing its job's row if one is stored.
    pub fn replace(&self, row: &StoredResult) -> Result<(), StoreError> {
        self.upgrade()?;
        let tx = self.sql(self.conn.unchecked_transaction())?;
        self.sql(tx.execute("DELETE FROM results WHERE job_id = ?1", [&row.job_id]))?;
        self.insert_row(&tx, row, unix_now_s(), false)?;
        self.sql(tx.commit())
    }

    /// Ids of the stored jobs that failed (what `run --retry-failed` runs again).
    pub fn failed_ids(&self) -> Result<BTreeSet<String>, StoreError> {
        let mut st = self.sql(
            self.conn
                .prepare("SELECT job_id FROM results WHERE status = 'failed'"),
        )?;
        let rows = self.sql(st.query_map([], |r| r.get::<_, String>(0)))?;
        let mut out = BTreeSet::new();
        for r in rows {
            out.insert(self.sql(r)?);
        }
        Ok(out)
    }

    /// Ids of every stored job.
    pub fn stored_ids(&self) -> Result<BTreeSet<String>, StoreError> {
        let mut st = self.sql(self.conn.prepare("SELECT job_id FROM results"))?;
        let rows = self.sql(st.query_map([], |r| r.get::<_, String>(0)))?;
        let mut out = BTreeSet::new();
        for r in rows {
            out.insert(self.sql(r)?);
        }
        Ok(out)
    }

    /// Every stored result, ordered by building, label, seed, each checked and its contents
    /// decoded ([`decode_row`]): a row changed outside floorcast is an error naming its job and
    /// field, never a silent failure.
    pub fn all(&self) -> Result<Vec<StoredResult>, StoreError> {
        // Stores of earlier builds have no stderr column (read as none; nothing is added to a
        // store read).
        let stderr = if self.has_column("results", "stderr_tail")? {
            "stderr_tail"
        } else {
            "NULL"
        };
        let mut st = self.sql(self.conn.prepare(&format!(
            "SELECT job_id, grid, building, building_hash, strategy, label, seed, settings_json, status,
                    error, summary_json, progress_csv, worker, wall_time_s, floorcast_version, {stderr}
             FROM results ORDER BY building, label, seed, job_id",
        )))?;
        let rows = self.sql(st.query_map([], |r| {
            // A value of the wrong type is the row's problem, named with its job.
            let id = r.get::<_, String>(0).unwrap_or_default();
            Ok(read_row(r).map_err(|e| (id, e)))
        }))?;
        let mut out = Vec::new();
        for r in rows {
            let tampered = |job: &str, what: &str, problem: String| StoreError::Row {
                path: self.path.clone(),
                problem: format!(
                    "job {}{what}: {problem}; the row was changed outside floorcast: restore the \
                     store from a copy, or delete the row to run the job again",
                    floorcast_worker::text::excerpt(job),
                ),
            };
            let (seed, raw) = match self.sql(r)? {
                Ok(read) => read,
                // An unknown status says what it is.
                Err((job, rusqlite::Error::FromSqlConversionFailure(8, _, e))) => {
                    return Err(tampered(&job, "", e.to_string()))
                }
                Err((job, e)) => {
                    return Err(tampered(
                        &job,
                        "",
                        format!("a value of the wrong type ({e})"),
                    ))
                }
            };
            // Seeds are u64, stored as SQLite's i64 by their bits (`seed as i64`): read back
            // the same way, 2^64-1 (stored as -1) included.
            let seed = seed as u64;
            let what = format!(
                " ({}, {}, seed {seed})",
                floorcast_worker::text::excerpt(&raw.row.building),
                floorcast_worker::text::excerpt(&raw.row.label),
            );
            let job = raw.row.job_id.clone();
            let tampered = |problem: String| tampered(&job, &what, problem);
            out.push(decode_row(raw, seed).map_err(tampered)?);
        }
        Ok(out)
    }

    /// Stores the tests of a sequential grid's batch (the path of each test statistic; a test
    /// replayed after a restart replaces its equal).
    pub fn record_tests(
        &self,
        grid: &str,
        tests: &[floorcast_stats::sprt::LabelTest],
    ) -> Result<(), StoreError> {
        let tx = self.sql(self.conn.unchecked_transaction())?;
        for t in tests {
            let s = &t.state;
            self.sql(tx.execute(
                "INSERT OR REPLACE INTO sequential (grid, label, reference, through_seed, pairs, mean,
                    variance, llr, lower, upper, decision)
                 VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ?11)",
                params![
                    grid,
                    t.label,
                    t.reference,
                    t.through_seed as i64,
                    s.pairs as i64,
                    s.mean,
                    s.variance,
                    s.llr,
                    s.lower,
                    s.upper,
                    s.decision.as_str()
                ],
            ))?;
        }
        self.sql(tx.commit())
    }

    /// Whether the store has table `name` (stores of earlier builds may lack the newer ones).
    fn has_table(&self, name: &str) -> Result<bool, StoreError> {
        let n: i64 = self.sql(self.conn.query_row(
            "SELECT count(*) FROM sqlite_master WHERE type = 'table' AND name = ?1",
            [name],
            |r| r.get(0),
        ))?;
        Ok(n > 0)
    }

    /// The stored tests of sequential grids, by grid, label and batch.
    pub fn tests(&self) -> Result<Vec<(String, floorcast_stats::sprt::LabelTest)>, StoreError> {
        use floorcast_stats::sprt::{LabelTest, SprtState};
        if !self.has_table("sequential")? {
            return Ok(Vec::new());
        }
        let mut st = self.sql(self.conn.prepare(
            "SELECT grid, label, reference, through_seed, pairs, mean, variance, llr, lower, upper,
                    decision
             FROM sequential ORDER BY grid, label, through_seed",
        ))?;
        let rows = self.sql(st.query_map([], |r| {
            let DecisionColumn(decision) = r.get(10)?;
            Ok((
                r.get::<_, String>(0)?,
                LabelTest {
                    label: r.get(1)?,
                    reference: r.get(2)?,
                    through_seed: r.get::<_, i64>(3)? as u64,
                    state: SprtState {
                        pairs: r.get::<_, i64>(4)? as usize,
                        mean: r.get(5)?,
                        variance: r.get(6)?,
                        llr: r.get(7)?,
                        lower: r.get(8)?,
                        upper: r.get(9)?,
                        decision,
                    },
                },
            ))
        }))?;
        let mut out = Vec::new();
        for r in rows {
            out.push(self.sql(r)?);
        }
        Ok(out)
    }

    /// Records a grid's label order and coverage level (what `report` shows them by); a grid
    /// run again replaces its entry.
    pub fn record_grid(
        &self,
        grid: &str,
        labels: &[String],
        coverage: f64,
    ) -> Result<(), StoreError> {
        let labels_json = serde_json::to_string(labels).unwrap_or_default();
        // Made here, by the run that writes it, not when a store is opened: opening one to
        // read it changes nothing in it (stores of earlier builds have no such table).
        self.sql(self.conn.execute_batch(
            "CREATE TABLE IF NOT EXISTS grids (
                grid TEXT PRIMARY KEY,
                labels_json TEXT NOT NULL,
                coverage REAL NOT NULL
             );",
        ))?;
        self.sql(self.conn.execute(
            "INSERT INTO grids (grid, labels_json, coverage) VALUES (?1, ?2, ?3)
             ON CONFLICT(grid) DO UPDATE SET labels_json = ?2, coverage = ?3",
            params![grid, labels_json, coverage],
        ))?;
        Ok(())
    }

    /// The grids recorded, in the order first recorded: name, labels in the grid's order,
    /// coverage level. Stores written before grids were recorded have none.
    pub fn grids(&self) -> Result<Vec<(String, Vec<String>, f64)>, StoreError> {
        if !self.has_table("grids")? {
            return Ok(Vec::new());
        }
        let mut st = self.sql(
            self.conn
                .prepare("SELECT grid, labels_json, coverage FROM grids ORDER BY rowid"),
        )?;
        let rows = self.sql(st.query_map([], |r| {
            Ok((
                r.get::<_, String>(0)?,
                r.get::<_, String>(1)?,
                r.get::<_, f64>(2)?,
            ))
        }))?;
        let mut out = Vec::new();
        for r in rows {
            let (grid, labels, coverage) = self.sql(r)?;
            let labels: Vec<String> =
                serde_json::from_str(&labels).map_err(|e| StoreError::Row {
                    path: self.path.clone(),
                    problem: format!("grid '{grid}': labels_json is not a list of labels ({e})"),
                })?;
            out.push((grid, labels, coverage));
        }
        Ok(out)
    }

    /// Stores a building's known-map tour under its building hash, start and key (replacing
    /// one stored under the same).
    pub fn record_tour(&self, t: &TourRecord) -> Result<(), StoreError> {
        // Made by the run that writes it, as `grids`: opening a store to read it changes nothing.
        self.sql(self.conn.execute_batch(
            "CREATE TABLE IF NOT EXISTS tours (
                building_hash TEXT NOT NULL,
                start_json TEXT NOT NULL,
                key_json TEXT NOT NULL,
                tour_json TEXT NOT NULL,
                PRIMARY KEY (building_hash, start_json, key_json)
             );",
        ))?;
        let start = serde_json::to_string(&t.start).unwrap_or_default();
        let tour = serde_json::to_string(t).unwrap_or_default();
        self.sql(self.conn.execute(
            "INSERT INTO tours (building_hash, start_json, key_json, tour_json) VALUES (?1, ?2, ?3, ?4)
             ON CONFLICT(building_hash, start_json, key_json) DO UPDATE SET tour_json = ?4",
            params![t.building_hash, start, t.key.text(), tour],
        ))?;
        Ok(())
    }

    /// The stored tours, each decoded and checked ([`TourRecord::validate`]); stores written
    /// before tours were stored have none.
    pub fn tours(&self) -> Result<Vec<TourRecord>, StoreError> {
        if !self.has_table("tours")? {
            return Ok(Vec::new());
        }
        let mut st = self.sql(self.conn.prepare(
            "SELECT building_hash, tour_json FROM tours ORDER BY building_hash, start_json, key_json",
        ))?;
        let rows =
            self.sql(st.query_map([], |r| Ok((r.get::<_, String>(0)?, r.get::<_, String>(1)?))))?;
        let mut out = Vec::new();
        for r in rows {
            let (hash, text) = self.sql(r)?;
            let bad = |problem: String| StoreError::Row {
                path: self.path.clone(),
                problem: format!("the tour of building {hash}: {problem}"),
            };
            let t: TourRecord = serde_json::from_str(&text)
                .map_err(|e| bad(format!("tour_json is not a tour record ({e})")))?;
            t.validate().map_err(bad)?;
            if t.building_hash != hash {
                return Err(bad(format!("tour_json is of building {}", t.building_hash)));
            }
            out.push(t);
        }
        Ok(out)
    }

    /// Every recorded failure, ordered by building, label, seed, job and attempt, each checked
    /// as read (a row changed outside floorcast is an error naming it). Stores written before
    /// failures were recorded have none (their failed rows are in [`Store::all`]).
    pub fn failures(&self) -> Result<Vec<Failure>, StoreError> {
        if !self.has_table("failures")? {
            return Ok(Vec::new());
        }
        let mut st = self.sql(self.conn.prepare(
            "SELECT job_id, attempt, grid, building, strategy, label, seed, error, stderr_tail,
                    worker, wall_time_s, floorcast_version, stored_unix_s
             FROM failures ORDER BY building, label, seed, job_id, attempt",
        ))?;
        let rows = self.sql(st.query_map([], |r| {
            Ok((
                r.get::<_, i64>(1)?,
                r.get::<_, i64>(6)?,
                Failure {
                    job_id: r.get(0)?,
                    attempt: 0,
                    grid: r.get(2)?,
                    building: r.get(3)?,
                    strategy: r.get(4)?,
                    label: r.get(5)?,
                    seed: 0,
                    error: r.get(7)?,
                    stderr_tail: r.get(8)?,
                    worker: r.get(9)?,
                    wall_time_s: r.get(10)?,
                    floorcast_version: r.get(11)?,
                    stored_unix_s: r.get(12)?,
                },
            ))
        }))?;
        let mut out = Vec::new();
        for r in rows {
            let (attempt, seed, mut f) = self.sql(r)?;
            let bad = |what: String| StoreError::Row {
                path: self.path.clone(),
                problem: format!(
                    "failure of job {}: {what}; the row was changed outside floorcast",
                    floorcast_worker::text::excerpt(&f.job_id)
                ),
            };
            f.attempt = u32::try_from(attempt)
                .ok()
                .filter(|a| *a >= 1)
                .ok_or_else(|| bad(format!("field attempt is {attempt}, expected 1 or more")))?;
            // By its bits, as it was stored (`seed as i64`).
            f.seed = seed as u64;
            if !(f.wall_time_s.is_finite() && f.wall_time_s >= 0.0) {
                return Err(bad(format!(
                    "field wall_time_s is {}, expected a finite number of seconds, 0 or more",
                    f.wall_time_s
                )));
            }
            out.push(f);
        }
        Ok(out)
    }

    pub fn record_run(&self, p: &Provenance) -> Result<(), StoreError> {
        self.upgrade()?;
        self.sql(self.conn.execute(
            "INSERT INTO runs (grid, command, git_commit, git_dirty, rustc, host, floorcast_version,
                started_unix_s, build_profile, cwd_git_commit, cwd_git_dirty)
             VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ?11)",
            params![p.grid, p.command, p.git_commit, p.git_dirty as i64, p.rustc, p.host, p.floorcast_version,
                p.started_unix_s, p.build_profile, p.cwd_git_commit, p.cwd_git_dirty as i64],
        ))?;
        Ok(())
    }
}

/// Columns added since the first layout (table, column, type), added to a store that lacks them
/// when it is opened to be written: a store of an earlier build stays readable and writable.
const ADDED_COLUMNS: [(&str, &str, &str); 4] = [
    ("results", "stderr_tail", "TEXT"),
    ("runs", "build_profile", "TEXT"),
    ("runs", "cwd_git_commit", "TEXT"),
    ("runs", "cwd_git_dirty", "INTEGER"),
];

/// A row of the results table as SQLite holds it: its text columns not yet decoded (`row` holds
/// the rest, its contents empty).
#[derive(Debug)]
pub struct RawRow {
    pub row: StoredResult,
    pub settings_json: String,
    pub summary_json: Option<String>,
    pub progress_csv: Option<String>,
}

/// One row of the results table as read, its seed apart (checked by the caller).
fn read_row(r: &rusqlite::Row<'_>) -> rusqlite::Result<(i64, RawRow)> {
    let row = StoredResult {
        job_id: r.get(0)?,
        grid: r.get(1)?,
        building: r.get(2)?,
        building_hash: r.get(3)?,
        strategy: r.get(4)?,
        label: r.get(5)?,
        seed: 0,
        settings: Settings::default(),
        status: {
            let word: String = r.get(8)?;
            JobStatus::parse(&word).ok_or_else(|| {
                rusqlite::Error::FromSqlConversionFailure(
                    8,
                    rusqlite::types::Type::Text,
                    format!(
                        "field status is '{}', expected ok or failed",
                        floorcast_worker::text::excerpt(&word)
                    )
                    .into(),
                )
            })?
        },
        error: r.get(9)?,
        summary: None,
        progress: None,
        worker: r.get(12)?,
        wall_time_s: r.get(13)?,
        floorcast_version: r.get(14)?,
        stderr_tail: r.get(15)?,
    };
    Ok((
        r.get::<_, i64>(6)?,
        RawRow {
            row,
            settings_json: r.get(7)?,
            summary_json: r.get(10)?,
            progress_csv: r.get(11)?,
        },
    ))
}

/// A stored row with its seed (checked by the caller), decoded: what it must hold is a status of
/// `ok` with a valid run summary of the row's seed and building
/// ([`RunSummary::from_json`](floorcast_worker::RunSummary::from_json)), or `failed` with its
/// error; settings that are a JSON object of settings (those it lacks at their defaults); a
/// progress curve, if any, that [`floorcast_stats::progress::decode`] reads; a finite wall time. The
/// error names the field.
pub fn decode_row(raw: RawRow, seed: u64) -> Result<StoredResult, String> {
    let RawRow {
        mut row,
        settings_json,
        summary_json,
        progress_csv,
    } = raw;
    row.seed = seed;
    if !(row.wall_time_s.is_finite() && row.wall_time_s >= 0.0) {
        return Err(format!(
            "field wall_time_s is {}, expected a finite number of seconds, 0 or more",
            row.wall_time_s
        ));
    }
    row.settings = decode_settings(&settings_json)?;
    if row.status == JobStatus::Ok && summary_json.is_none() {
        return Err("field summary_json is empty, expected the run's summary".into());
    }
    if let Some(text) = summary_json {
        row.summary = Some(decode_summary(&text, &row)?);
    }
    if row.status == JobStatus::Failed && row.error.as_deref().is_none_or(|e| e.trim().is_empty()) {
        return Err("field error is empty, expected why the job failed".into());
    }
    if let Some(text) = progress_csv {
        row.progress = Some(floorcast_stats::progress::decode(&text).map_err(|e| {
            format!(
                "field progress_csv: {}",
                floorcast_worker::text::shown(&e, 200)
            )
        })?);
    }
    Ok(row)
}

/// A run as an export file holds it (`board.rs`): `row` (its seed apart, and its settings,
/// summary and curve empty) with its settings and summary as JSON and its curve as the store's
/// CSV, decoded and checked as a stored row is ([`decode_row`]).
pub fn decode_exported(
    row: StoredResult,
    seed: u64,
    settings: &serde_json::Value,
    summary: &serde_json::Value,
    progress: String,
) -> Result<StoredResult, String> {
    let raw = RawRow {
        row,
        settings_json: settings.to_string(),
        summary_json: Some(summary.to_string()),
        progress_csv: Some(progress),
    };
    decode_row(raw, seed)
}

/// A row's settings from its `settings_json`: a JSON object of settings, each one it lacks at
/// its default (`layout_update_fraction` at 0, with which a row without it was made).
fn decode_settings(text: &str) -> Result<Settings, String> {
    match serde_json::from_str::<serde_json::Value>(text) {
        Ok(v @ serde_json::Value::Object(_)) => serde_json::from_value(v).map_err(|e| {
            format!(
                "field settings_json: {}",
                floorcast_worker::text::shown(&e.to_string(), 200)
            )
        }),
        _ => Err("field settings_json is not a JSON object".into()),
    }
}

/// A row's run summary from its `summary_json`, checked against the row's seed and building.
fn decode_summary(text: &str, row: &StoredResult) -> Result<RunSummary, String> {
    let s = RunSummary::from_json(text).map_err(|e| {
        format!(
            "field summary_json: {}",
            floorcast_worker::text::shown(&e, 200)
        )
    })?;
    if s.seed != row.seed {
        return Err(format!(
            "field summary_json.seed is {}, the row's seed is {}",
            s.seed, row.seed
        ));
    }
    if s.building_hash != row.building_hash {
        return Err("field summary_json.building_hash differs from the row's building_hash".into());
    }
    Ok(s)
}

/// Seconds since the Unix epoch (when a row was stored).
fn unix_now_s() -> f64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_secs_f64())
        .unwrap_or(0.0)
}

pub fn host_name() -> String {
    std::fs::read_to_string("/etc/hostname")
        .ok()
        .map(|s| s.trim().to_string())
        .filter(|s| !s.is_empty())
        .or_else(|| std::env::var("HOSTNAME").ok())
        .unwrap_or_else(|| "unknown".into())
}

/// Provenance of this process: floorcast's own build (`build`: commit, dirty flag, profile),
/// the commit and dirty flag of the current directory's repository (or "none"), compiler, host,
/// version.
pub fn provenance(grid: &str, command: &str, build: &BuildInfo) -> Provenance {
    let git = |args: &[&str]| {
        std::process::Command::new("git")
            .args(args)
            .stderr(std::process::Stdio::null())
            .output()
            .ok()
            .filter(|o| o.status.success())
            .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
    };
    let cwd_git_commit = git(&["rev-parse", "HEAD"]).unwrap_or_else(|| "none".into());
    let cwd_git_dirty =
        git(&["status", "--porcelain", "--untracked-files=no"]).is_some_and(|s| !s.is_empty());
    let host = host_name();
    Provenance {
        grid: grid.to_string(),
        command: command.to_string(),
        git_commit: build.git_commit.clone(),
        git_dirty: build.git_dirty,
        build_profile: build.profile.clone(),
        cwd_git_commit,
        cwd_git_dirty,
        rustc: env!("FLOORCAST_RUSTC_VERSION").to_string(),
        host,
        floorcast_version: floorcast_worker::FLOORCAST_VERSION.to_string(),
        started_unix_s: std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map(|d| d.as_secs_f64())
            .unwrap_or(0.0),
    }
}

/// The `sequential.decision` column: the words `Decision::as_str` writes, decoded by
/// `Decision`'s serde codec (a word it does not know is an error naming it).
struct DecisionColumn(floorcast_stats::sprt::Decision);

impl rusqlite::types::FromSql for DecisionColumn {
    fn column_result(v: rusqlite::types::ValueRef<'_>) -> rusqlite::types::FromSqlResult<Self> {
        use serde::de::IntoDeserializer;
        use serde::Deserialize;
        let word: serde::de::value::StrDeserializer<'_, serde::de::value::Error> =
            v.as_str()?.into_deserializer();
        floorcast_stats::sprt::Decision::deserialize(word)
            .map(DecisionColumn)
            .map_err(|e| rusqlite::types::FromSqlError::Other(Box::new(e)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(id: &str) -> StoredResult {
        StoredResult {
            job_id: id.into(),
            grid: "g".into(),
            building: "b".into(),
            building_hash: "h".into(),
            strategy: "baseline".into(),
            label: "baseline".into(),
            seed: 1,
            settings: Settings::default(),
            status: JobStatus::Failed,
            error: Some("no free space at the start".into()),
            summary: None,
            progress: Some(vec![floorcast_stats::progress::Sample::from([
                0.0, 0.0, 0.0,
            ])]),
            worker: "local-0".into(),
            wall_time_s: 1.0,
            floorcast_version: "0".into(),
            stderr_tail: None,
        }
    }

    /// The files of `dir`, by name.
    fn files_in(dir: &Path) -> Vec<String> {
        let mut names: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        names
    }

    /// A store of one ok row (a real summary) and one failed row, closed (its log merged).
    fn good_store(dir: &Path) {
        let s = Store::open(dir).unwrap();
        let mut ok = floorcast_stats::fixtures::stored("b", "baseline", 1, 600.0);
        ok.building_hash = "bd6183b04c0805da57279aa53b7844c1".into();
        s.insert_many(&[ok, row("failed-job")]).unwrap();
    }

    /// Every seed, 2^64-1 included (SQLite's integers are i64: it is stored as -1), reads back
    /// as itself, in results and failures alike.
    #[test]
    fn seeds_are_stored_losslessly() {
        let dir = tempfile::tempdir().unwrap();
        let s = Store::open(dir.path()).unwrap();
        let seeds = [
            0,
            1,
            i64::MAX as u64,
            i64::MAX as u64 + 1,
            u64::MAX - 1,
            u64::MAX,
        ];
        let rows: Vec<StoredResult> = seeds
            .iter()
            .map(|&seed| StoredResult {
                seed,
                ..row(&format!("failed-{seed}"))
            })
            .collect();
        s.insert_many(&rows).unwrap();
        let mut got: Vec<u64> = s.all().unwrap().iter().map(|r| r.seed).collect();
        got.sort_unstable();
        assert_eq!(got, seeds);
        let mut failed: Vec<u64> = s.failures().unwrap().iter().map(|f| f.seed).collect();
        failed.sort_unstable();
        assert_eq!(failed, seeds);
    }

    /// Overwrites `len` bytes of `path` at `at` with pseudo-random bytes.
    fn scribble(path: &Path, at: u64, len: usize) {
        use std::io::{Seek, Write};
        let mut f = std::fs::OpenOptions::new().write(true).open(path).unwrap();
        f.seek(std::io::SeekFrom::Start(at)).unwrap();
        let bytes: Vec<u8> = (0..len).map(|i| (i * 7919 % 251) as u8).collect();
        f.write_all(&bytes).unwrap();
    }

    #[test]
    #[allow(clippy::too_many_lines)] // a table of cases
    fn damaged_and_foreign_stores_are_told_apart_and_left_untouched() {
        // (what is at results.sqlite, how it is made, words of the message)
        type Make = fn(&Path);
        let cases: &[(&str, Make, &[&str])] = &[
            (
                "empty file",
                |d| std::fs::write(d.join(DB_FILE), b"").unwrap(),
                &["is damaged", "an empty file"],
            ),
            (
                "text file",
                |d| {
                    std::fs::write(d.join(DB_FILE), "hello, not a database at all.\n".repeat(9))
                        .unwrap()
                },
                &["is not a floorcast results store", "not an SQLite database"],
            ),
            (
                "random bytes where a run has run",
                |d| {
                    good_store(d);
                    std::fs::write(d.join(LOCK_FILE), b"").unwrap();
                    scribble(&d.join(DB_FILE), 0, 4096);
                },
                &["is damaged", "not SQLite's header"],
            ),
            (
                "directory",
                |d| std::fs::create_dir(d.join(DB_FILE)).unwrap(),
                &["is not a floorcast results store", "not a regular file"],
            ),
            (
                "foreign sqlite",
                |d| {
                    let c = Connection::open(d.join(DB_FILE)).unwrap();
                    c.execute_batch(
                        "CREATE TABLE notes (x TEXT); INSERT INTO notes VALUES ('mine');",
                    )
                    .unwrap();
                },
                &[
                    "is not a floorcast results store",
                    "without floorcast's tables",
                ],
            ),
            (
                "truncated store",
                |d| {
                    good_store(d);
                    let p = d.join(DB_FILE);
                    let len = std::fs::metadata(&p).unwrap().len();
                    let f = std::fs::OpenOptions::new().write(true).open(&p).unwrap();
                    f.set_len(len / 2).unwrap();
                },
                &["is damaged", "malformed", ".recover"],
            ),
            (
                "bytes scribbled over its pages",
                |d| {
                    good_store(d);
                    scribble(&d.join(DB_FILE), 100, 8000);
                },
                &["is damaged"],
            ),
            (
                "results table dropped",
                |d| {
                    good_store(d);
                    Connection::open(d.join(DB_FILE))
                        .unwrap()
                        .execute_batch("DROP TABLE results")
                        .unwrap();
                },
                &["is damaged", "its results table is missing"],
            ),
            (
                "another layout version",
                |d| {
                    good_store(d);
                    Connection::open(d.join(DB_FILE))
                        .unwrap()
                        .execute_batch("UPDATE meta SET value = '99' WHERE key = 'store_version'")
                        .unwrap();
                },
                &["layout version 99"],
            ),
        ];
        for (what, make, words) in cases {
            let dir = tempfile::tempdir().unwrap();
            make(dir.path());
            let p = dir.path().join(DB_FILE);
            let before = std::fs::read(&p).ok();
            let files = files_in(dir.path());
            for (how, r) in [
                ("open", Store::open(dir.path())),
                ("open_existing", Store::open_existing(dir.path())),
            ] {
                let e = r.unwrap_err().to_string();
                for w in *words {
                    assert!(e.contains(w), "{what}, {how}: {w:?} missing in: {e}");
                }
                assert_eq!(
                    std::fs::read(&p).ok(),
                    before,
                    "{what} was changed by {how}"
                );
                assert_eq!(files_in(dir.path()), files, "{what}: {how} made files");
            }
        }
    }

    #[test]
    fn reading_a_store_creates_nothing_beside_it() {
        let dir = tempfile::tempdir().unwrap();
        good_store(dir.path());
        let files = files_in(dir.path());
        assert_eq!(files, vec![DB_FILE.to_string()]);
        let before = std::fs::read(dir.path().join(DB_FILE)).unwrap();
        let s = Store::open_existing(dir.path()).unwrap();
        assert_eq!(s.all().unwrap().len(), 2);
        assert!(s.tests().unwrap().is_empty());
        assert!(s.grids().unwrap().is_empty());
        drop(s);
        assert_eq!(files_in(dir.path()), files);
        assert_eq!(std::fs::read(dir.path().join(DB_FILE)).unwrap(), before);
    }

    #[test]
    fn a_store_another_program_holds_is_called_locked() {
        let dir = tempfile::tempdir().unwrap();
        good_store(dir.path());
        let holder = Connection::open(dir.path().join(DB_FILE)).unwrap();
        holder
            .execute_batch(
                "PRAGMA locking_mode = EXCLUSIVE; BEGIN EXCLUSIVE; \
                 INSERT INTO meta (key, value) VALUES ('held', 'yes');",
            )
            .unwrap();
        for (how, r) in [
            ("open", Store::open(dir.path())),
            ("open_existing", Store::open_existing(dir.path())),
        ] {
            let e = r.unwrap_err().to_string();
            assert!(
                e.contains("is locked by another program") && e.contains("try again"),
                "{how}: {e}"
            );
        }
    }

    #[test]
    fn sqlite_errors_are_classified() {
        let dir = tempfile::tempdir().unwrap();
        good_store(dir.path());
        let p = dir.path().join(DB_FILE);
        let ro =
            Connection::open_with_flags(&p, rusqlite::OpenFlags::SQLITE_OPEN_READ_ONLY).unwrap();
        let e = ro
            .execute("INSERT INTO meta (key, value) VALUES ('k', 'v')", [])
            .unwrap_err();
        assert!(matches!(classify(&p, e), StoreError::ReadOnly { .. }));
        let e = ro.execute("SELECT nonsense FROM nowhere", []).unwrap_err();
        assert!(matches!(classify(&p, e), StoreError::Sql { .. }));
    }

    #[test]
    fn a_tampered_row_is_an_error_naming_its_job_and_field() {
        // (the change, words of the message)
        let cases: &[(&str, &[&str])] = &[
            (
                "UPDATE results SET summary_json = 'not json' WHERE status = 'ok'",
                &["summary_json", "not JSON"],
            ),
            (
                "UPDATE results SET summary_json = json_set(summary_json, '$.explored_fraction', 7) WHERE status = 'ok'",
                &["explored_fraction is 7", "[0, 1]"],
            ),
            (
                "UPDATE results SET summary_json = json_set(summary_json, '$.version', 99) WHERE status = 'ok'",
                &["summary_json", "version 99"],
            ),
            (
                "UPDATE results SET summary_json = json_set(summary_json, '$.total_time_s', -5) WHERE status = 'ok'",
                &["total_time_s is -5"],
            ),
            (
                "UPDATE results SET summary_json = json_set(summary_json, '$.seed', 2) WHERE status = 'ok'",
                &["summary_json.seed is 2"],
            ),
            (
                "UPDATE results SET summary_json = json_set(summary_json, '$.end_reason', 'meteor') WHERE status = 'ok'",
                &["field summary_json", "end_reason 'meteor'"],
            ),
            (
                "UPDATE results SET summary_json = NULL WHERE status = 'ok'",
                &["summary_json is empty"],
            ),
            (
                "UPDATE results SET status = 'great' WHERE status = 'ok'",
                &["field status is 'great'"],
            ),
            (
                "UPDATE results SET error = NULL WHERE status = 'failed'",
                &["failed-job", "field error is empty"],
            ),
            (
                "UPDATE results SET wall_time_s = 1e999 WHERE status = 'failed'",
                &["wall_time_s is inf"],
            ),
            (
                "UPDATE results SET settings_json = '[1]' WHERE status = 'failed'",
                &["settings_json is not a JSON object"],
            ),
            (
                "UPDATE results SET settings_json = '{\"alpah\": 0.3}' WHERE status = 'failed'",
                &["field settings_json", "unknown field `alpah`"],
            ),
            (
                "UPDATE results SET settings_json = '{\"alpha\": \"high\"}' WHERE status = 'ok'",
                &["field settings_json", "invalid type"],
            ),
            (
                "UPDATE results SET progress_csv = 'time_s,explored_area_m2,explored_fraction\n1.0,2.0' WHERE status = 'failed'",
                &["field progress_csv", "line 2 is not three numbers"],
            ),
            (
                "UPDATE results SET progress_csv = '' WHERE status = 'failed'",
                &["field progress_csv", "empty"],
            ),
            (
                "UPDATE results SET wall_time_s = 'slow' WHERE status = 'failed'",
                &["wrong type"],
            ),
        ];
        for (change, words) in cases {
            let dir = tempfile::tempdir().unwrap();
            good_store(dir.path());
            Connection::open(dir.path().join(DB_FILE))
                .unwrap()
                .execute_batch(change)
                .unwrap();
            for (how, s) in [
                ("open", Store::open(dir.path()).unwrap()),
                ("open_existing", Store::open_existing(dir.path()).unwrap()),
            ] {
                let e = s.all().unwrap_err().to_string();
                for w in words.iter().chain(&["job ", "changed outside floorcast"]) {
                    assert!(e.contains(w), "{change}, {how}: {w:?} missing in: {e}");
                }
            }
        }
        // Untouched, both rows read back.
        let dir = tempfile::tempdir().unwrap();
        good_store(dir.path());
        assert_eq!(
            Store::open_existing(dir.path())
                .unwrap()
                .all()
                .unwrap()
                .len(),
            2
        );
    }

    #[test]
    fn inserts_once_and_survives_reopening() {
        let dir = tempfile::tempdir().unwrap();
        {
            let s = Store::open(dir.path()).unwrap();
            assert!(s.insert(&row("a")).unwrap());
            assert!(!s.insert(&row("a")).unwrap(), "duplicate is ignored");
            assert!(s.insert(&row("b")).unwrap());
            assert_eq!(s.insert_many(&[row("b"), row("c"), row("d")]).unwrap(), 2);
        }
        let s = Store::open(dir.path()).unwrap();
        assert_eq!(s.stored_ids().unwrap().len(), 4);
        assert_eq!(s.all().unwrap()[0], row("a"));
    }

    /// A row reads back as it was written, its contents typed, and is written as before: the
    /// settings, summary and progress curve as their JSON and CSV.
    #[test]
    fn contents_are_typed_and_written_as_before() {
        let dir = tempfile::tempdir().unwrap();
        good_store(dir.path());
        let s = Store::open_existing(dir.path()).unwrap();
        let mut ok = floorcast_stats::fixtures::stored("b", "baseline", 1, 600.0);
        ok.building_hash = "bd6183b04c0805da57279aa53b7844c1".into();
        assert_eq!(s.all().unwrap(), vec![ok.clone(), row("failed-job")]);
        let text: (String, String, Option<String>) = s
            .conn
            .query_row(
                "SELECT settings_json, summary_json, progress_csv FROM results WHERE status = 'failed'",
                [],
                |r| Ok((r.get(0)?, r.get::<_, Option<String>>(1)?.unwrap_or_default(), r.get(2)?)),
            )
            .unwrap();
        assert_eq!(text.0, serde_json::to_string(&Settings::default()).unwrap());
        assert_eq!(text.1, "");
        assert_eq!(
            text.2.as_deref(),
            Some("time_s,explored_area_m2,explored_fraction\n0.0,0.000,0.00000\n")
        );
        let summary: String = s
            .conn
            .query_row(
                "SELECT summary_json FROM results WHERE status = 'ok'",
                [],
                |r| r.get(0),
            )
            .unwrap();
        assert_eq!(summary, serde_json::to_string(&ok.summary).unwrap());
    }

    /// A row written before a setting existed reads with that setting at its default, but for
    /// `layout_update_fraction`, whose default changed (0, the paper's, to 0.1 in 0.7): a row
    /// without it was made with 0.
    #[test]
    fn settings_a_row_lacks_are_at_their_defaults() {
        let dir = tempfile::tempdir().unwrap();
        good_store(dir.path());
        Connection::open(dir.path().join(DB_FILE))
            .unwrap()
            .execute_batch("UPDATE results SET settings_json = '{\"alpha\": 0.7}'")
            .unwrap();
        for r in Store::open_existing(dir.path()).unwrap().all().unwrap() {
            let want = Settings {
                alpha: 0.7,
                layout_update_fraction: 0.0,
                ..Settings::default()
            };
            assert_eq!(r.settings, want, "{}", r.job_id);
        }
    }

    /// Every failure is recorded with its attempt number; a row is replaced only for a job
    /// retried, and only when its stored row failed; the failures it replaces stay.
    #[test]
    fn failures_are_kept_when_a_retried_job_replaces_its_row() {
        let dir = tempfile::tempdir().unwrap();
        let s = Store::open(dir.path()).unwrap();
        let mut failed = row("j");
        failed.stderr_tail = Some("Traceback (most recent call last):\nValueError: x\n".into());
        let mut ok = floorcast_stats::fixtures::stored("b", "baseline", 1, 600.0);
        ok.job_id = "j".into();
        ok.building_hash = "bd6183b04c0805da57279aa53b7844c1".into();
        let retry: BTreeSet<String> = ["j".to_string()].into();
        // (row, retried, stored, status after, attempts recorded after)
        let steps = [
            (&failed, false, 1, JobStatus::Failed, 1),
            (&failed, false, 0, JobStatus::Failed, 1),
            (&ok, false, 0, JobStatus::Failed, 1),
            (&failed, true, 1, JobStatus::Failed, 2),
            (&ok, true, 1, JobStatus::Ok, 2),
            (&failed, true, 0, JobStatus::Ok, 2),
        ];
        for (i, (r, retried, stored, status, attempts)) in steps.into_iter().enumerate() {
            let set = if retried {
                retry.clone()
            } else {
                BTreeSet::new()
            };
            let n = s
                .insert_many_replacing(std::slice::from_ref(r), &set)
                .unwrap();
            assert_eq!(n, stored, "step {i}");
            assert_eq!(s.all().unwrap()[0].status, status, "step {i}");
            let f = s.failures().unwrap();
            assert_eq!(f.len(), attempts, "step {i}");
            assert_eq!(
                f.iter().map(|f| f.attempt).collect::<Vec<_>>(),
                (1..=attempts as u32).collect::<Vec<_>>()
            );
        }
        let f = &s.failures().unwrap()[1];
        assert_eq!(f.error, "no free space at the start");
        assert_eq!(f.stderr_tail, failed.stderr_tail);
        assert_eq!((f.building.as_str(), f.seed), ("b", 1));
        assert_eq!(s.failed_ids().unwrap().len(), 0);
    }

    /// A store written before failures, stderr and floorcast's own commit were recorded opens
    /// to be read as it is (nothing added), and to be written with the table and columns
    /// added; its failed row becomes the first attempt when the job is retried.
    #[test]
    fn a_store_of_the_earlier_layout_gains_the_new_table_and_columns() {
        let dir = tempfile::tempdir().unwrap();
        {
            let conn = Connection::open(dir.path().join(DB_FILE)).unwrap();
            conn.execute_batch(
                "CREATE TABLE meta (key TEXT PRIMARY KEY, value TEXT NOT NULL);
                 INSERT INTO meta VALUES ('store_version', '1');
                 CREATE TABLE results (job_id TEXT PRIMARY KEY, grid TEXT NOT NULL,
                    building TEXT NOT NULL, building_hash TEXT NOT NULL, strategy TEXT NOT NULL,
                    label TEXT NOT NULL, seed INTEGER NOT NULL, settings_json TEXT NOT NULL,
                    status TEXT NOT NULL, error TEXT, summary_json TEXT, progress_csv TEXT,
                    worker TEXT NOT NULL, wall_time_s REAL NOT NULL,
                    floorcast_version TEXT NOT NULL, stored_unix_s REAL NOT NULL);
                 CREATE TABLE runs (id INTEGER PRIMARY KEY AUTOINCREMENT, grid TEXT NOT NULL,
                    command TEXT NOT NULL, git_commit TEXT NOT NULL, git_dirty INTEGER NOT NULL,
                    rustc TEXT NOT NULL, host TEXT NOT NULL, floorcast_version TEXT NOT NULL,
                    started_unix_s REAL NOT NULL);
                 INSERT INTO results VALUES ('j', 'g', 'b', 'h', 'baseline', 'baseline', 1, '{}',
                    'failed', 'it crashed', NULL, NULL, 'w', 2.0, '0.6.0', 5.0);",
            )
            .unwrap();
        }
        let read = Store::open_existing(dir.path()).unwrap();
        assert_eq!(read.all().unwrap()[0].stderr_tail, None);
        assert_eq!(read.failures().unwrap(), vec![]);
        assert!(!read.has_table("failures").unwrap());
        assert!(!read.has_column("runs", "cwd_git_commit").unwrap());
        drop(read);
        let s = Store::open(dir.path()).unwrap();
        // Opened to be written, it is changed by its first write only.
        assert!(!s.has_table("failures").unwrap());
        assert!(!s.has_column("results", "stderr_tail").unwrap());
        let build = BuildInfo {
            git_commit: "c".repeat(40),
            git_dirty: true,
            profile: "release".into(),
        };
        s.record_run(&provenance("g", "floorcast run g", &build))
            .unwrap();
        assert!(s.has_table("failures").unwrap());
        for (table, column, _) in ADDED_COLUMNS {
            assert!(s.has_column(table, column).unwrap(), "{table}.{column}");
        }
        let runs: (String, i64, String) = s
            .conn
            .query_row(
                "SELECT git_commit, git_dirty, build_profile FROM runs",
                [],
                |r| Ok((r.get(0)?, r.get(1)?, r.get(2)?)),
            )
            .unwrap();
        assert_eq!(runs, ("c".repeat(40), 1, "release".to_string()));
        let mut again = row("j");
        again.error = Some("it crashed again".into());
        let retry: BTreeSet<String> = ["j".to_string()].into();
        assert_eq!(s.insert_many_replacing(&[again], &retry).unwrap(), 1);
        let f = s.failures().unwrap();
        let got: Vec<(u32, &str, f64)> = f
            .iter()
            .map(|f| (f.attempt, f.error.as_str(), f.stored_unix_s))
            .collect();
        assert_eq!(got[0], (1, "it crashed", 5.0));
        assert_eq!((got[1].0, got[1].1), (2, "it crashed again"));
    }

    /// A sequential test's decision is stored as its word (`Decision::as_str`) and read back
    /// by its serde codec; a word that is no decision is an error naming it.
    #[test]
    fn sequential_decisions_are_stored_as_words_and_read_back() {
        use floorcast_stats::sprt::{Decision, LabelTest, SprtState};
        let dir = tempfile::tempdir().unwrap();
        let s = Store::open(dir.path()).unwrap();
        let test = |label: &str, decision| LabelTest {
            label: label.into(),
            reference: "baseline".into(),
            through_seed: 4,
            state: SprtState {
                pairs: 4,
                mean: 0.25,
                variance: 0.5,
                llr: 1.5,
                lower: -2.0,
                upper: 3.0,
                decision,
            },
        };
        let tests = vec![
            test("a", Decision::H0),
            test("b", Decision::H1),
            test("c", Decision::Undecided),
        ];
        s.record_tests("g", &tests).unwrap();
        let read: Vec<LabelTest> = s.tests().unwrap().into_iter().map(|(_, t)| t).collect();
        assert_eq!(read, tests);
        let words: Vec<String> = s
            .conn
            .prepare("SELECT decision FROM sequential ORDER BY label")
            .unwrap()
            .query_map([], |r| r.get(0))
            .unwrap()
            .map(Result::unwrap)
            .collect();
        assert_eq!(words, ["H0", "H1", "undecided"]);
        s.conn
            .execute(
                "UPDATE sequential SET decision = 'maybe' WHERE label = 'c'",
                [],
            )
            .unwrap();
        let e = s.tests().unwrap_err().to_string();
        assert!(e.contains("unknown variant `maybe`"), "{e}");
    }
}
