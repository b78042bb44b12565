//! An external strategy's program as a job and its record carry it: its command, its files and
//! their hash (its identity), its timeout and parameters, and its files shipped to a remote
//! worker and written there ([`StrategyProgram::materialize`]).

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use serde_json::{Map, Value};

/// The default time a program has for each reply (s).
pub const DEFAULT_TIMEOUT_S: f64 = 10.0;
/// The largest `params` object (bytes of its JSON).
pub const MAX_PARAMS_BYTES: usize = 64 << 10;

/// An external strategy's program: how to start it and what it is, as a job and its record
/// carry it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StrategyProgram {
    /// The command, split into words (the first is the executable); words that name files
    /// are relative to `dir`.
    pub command: Vec<String>,
    /// Further files the program needs (relative to `dir`): hashed into its identity and sent
    /// to remote workers with the words of the command that name files.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub files: Vec<String>,
    /// SHA-256 (hex) over the program's files ([`StrategyProgram::file_names`]: their names as
    /// written and their contents): the program's identity (empty when it has none).
    pub files_sha256: String,
    /// Seconds the program has for each reply.
    pub timeout_s: f64,
    /// The strategy's own parameters, sent to it in the run message (`params`): part of its
    /// identity, so that one program with other parameters is another strategy.
    #[serde(default, skip_serializing_if = "Map::is_empty")]
    pub params: Map<String, Value>,
    /// Where the words and files are relative to (not part of the identity).
    #[serde(skip)]
    pub dir: PathBuf,
    /// Written from a remote job's contents, checked against `files_sha256` then (its words
    /// may have been moved: a file named by an absolute path is written inside the job's
    /// directory).
    #[serde(skip)]
    pub received: bool,
}

/// A program's files: each name as written and its bytes.
pub type ProgramFiles = Vec<(String, Vec<u8>)>;

/// Most files a program may have, and bytes in all (they travel with every remote job).
pub const MAX_PROGRAM_FILES: usize = 64;
pub const MAX_PROGRAM_BYTES: u64 = 8 << 20;

impl StrategyProgram {
    /// The program run by `command` (with further `files`), whose words that name files
    /// relative to `dir` are hashed into its identity with `files`. The command is not run.
    pub fn new(
        command: Vec<String>,
        files: Vec<String>,
        dir: &Path,
        timeout_s: f64,
    ) -> Result<Self, String> {
        if command.is_empty() || command[0].trim().is_empty() {
            return Err("the strategy command is empty (expected a program and its arguments, e.g. \"python3 my_strategy.py\")".into());
        }
        check_timeout(timeout_s)?;
        for f in &files {
            check_file(dir, f)?;
        }
        let mut p = Self {
            command,
            files,
            files_sha256: String::new(),
            timeout_s,
            params: Map::new(),
            dir: dir.to_path_buf(),
            received: false,
        };
        p.files_sha256 = p.hash_files()?;
        Ok(p)
    }

    /// Whether `other` is the same program as a record names it: the same command, files,
    /// their hash, timeout and parameters (where the files lie, `dir`, and whether they were
    /// received are not part of a program's identity: a record read back has neither).
    pub fn same_identity(&self, other: &StrategyProgram) -> bool {
        self.command == other.command
            && self.files == other.files
            && self.files_sha256 == other.files_sha256
            && self.timeout_s == other.timeout_s
            && self.params == other.params
    }

    /// The program with its own parameters (at most [`MAX_PARAMS_BYTES`] of JSON).
    pub fn with_params(mut self, params: Map<String, Value>) -> Result<Self, String> {
        let bytes = Value::Object(params.clone()).to_string().len();
        if bytes > MAX_PARAMS_BYTES {
            return Err(format!(
                "the strategy's params take {bytes} bytes of JSON (at most {MAX_PARAMS_BYTES}); pass large data as a file"
            ));
        }
        self.params = params;
        Ok(self)
    }

    /// The program from a command line split as a shell splits words.
    pub fn from_command_line(line: &str, dir: &Path, timeout_s: f64) -> Result<Self, String> {
        let words = shlex::split(line).ok_or_else(|| {
            format!(
                "cannot split the strategy command '{}' into words (an unclosed quote?)",
                crate::text::excerpt(line)
            )
        })?;
        Self::new(words, Vec::new(), dir, timeout_s)
    }

    /// The program's files, as written: the words of the command that name files (relative to
    /// `dir`), then `files`, each once.
    pub fn file_names(&self) -> Vec<String> {
        let mut names: Vec<String> = Vec::new();
        let words = self.command.iter().filter(|w| self.dir.join(w).is_file());
        for n in words.chain(&self.files) {
            if !names.contains(n) {
                names.push(n.clone());
            }
        }
        names
    }

    /// The files' contents, by name ([`StrategyProgram::file_names`]), size-checked.
    pub fn read_files(&self) -> Result<ProgramFiles, String> {
        let names = self.file_names();
        if names.len() > MAX_PROGRAM_FILES {
            return Err(format!(
                "the program has {} files, more than {MAX_PROGRAM_FILES}",
                names.len()
            ));
        }
        let mut total = 0u64;
        names
            .into_iter()
            .map(|n| {
                let path = self.dir.join(&n);
                total += std::fs::metadata(&path).map(|m| m.len()).unwrap_or(0);
                if total > MAX_PROGRAM_BYTES {
                    return Err(format!(
                        "the program's files reach {} with more than the {} MiB a program may have",
                        path.display(),
                        MAX_PROGRAM_BYTES >> 20
                    ));
                }
                let bytes = std::fs::read(&path)
                    .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
                Ok((n, bytes))
            })
            .collect()
    }

    fn hash_files(&self) -> Result<String, String> {
        Ok(files_sha256(&self.read_files()?))
    }

    /// Checks that the files are still the ones the identity was made of (a program received
    /// with a remote job was checked as it was written).
    pub fn check_files(&self) -> Result<(), String> {
        if self.received {
            return Ok(());
        }
        let now = self.hash_files()?;
        if now != self.files_sha256 {
            return Err(format!(
                "the program's files changed since the grid was planned (sha256 {}, expected {})",
                &now[..now.len().min(12)],
                &self.files_sha256[..self.files_sha256.len().min(12)]
            ));
        }
        Ok(())
    }

    /// The program with its files written under `root` (as a remote worker receives them),
    /// their relative layout kept; checked against `files_sha256`.
    pub fn materialize(
        command: Vec<String>,
        files: Vec<String>,
        contents: &[(String, Vec<u8>)],
        sha256: &str,
        timeout_s: f64,
        root: &Path,
    ) -> Result<Self, String> {
        if files_sha256(contents) != sha256 {
            return Err("the program's files arrived damaged (their hash differs)".into());
        }
        // A name may climb out of its directory ("../python/x.py"): the files go that many
        // levels below `root`, so that every name stays inside it. A file named by an absolute
        // path (on the coordinator's machine) goes to a directory of its own in `root`, and the
        // words naming it are moved there.
        let is_absolute = |name: &str| Path::new(name).is_absolute();
        let mut depth = 0;
        for (name, _) in contents.iter().filter(|(n, _)| !is_absolute(n)) {
            depth = depth.max(relative_parts(name)?.0);
        }
        let mut dir = root.to_path_buf();
        for i in 0..depth {
            dir.push(format!("d{i}"));
        }
        let mut moved: Vec<(String, String)> = Vec::new();
        for (i, (name, bytes)) in contents.iter().enumerate() {
            let path = if is_absolute(name) {
                let base = Path::new(name)
                    .file_name()
                    .ok_or_else(|| format!("file '{name}' names no file"))?;
                let p = root.join(format!("abs{i}")).join(base);
                moved.push((name.clone(), p.to_string_lossy().into_owned()));
                p
            } else {
                let (up, parts) = relative_parts(name)?;
                let mut path = dir.clone();
                for _ in 0..up {
                    path.pop();
                }
                path.extend(parts);
                path
            };
            if let Some(parent) = path.parent() {
                std::fs::create_dir_all(parent)
                    .map_err(|e| format!("cannot create {}: {e}", parent.display()))?;
            }
            std::fs::write(&path, bytes)
                .map_err(|e| format!("cannot write {}: {e}", path.display()))?;
        }
        std::fs::create_dir_all(&dir)
            .map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
        let moved_word = |w: String| {
            moved
                .iter()
                .find(|(from, _)| *from == w)
                .map_or(w.clone(), |(_, to)| to.clone())
        };
        Ok(Self {
            command: command.into_iter().map(moved_word).collect(),
            files: files.into_iter().map(moved_word).collect(),
            files_sha256: sha256.to_string(),
            timeout_s,
            params: Map::new(),
            dir,
            received: true,
        })
    }

    /// The command with its words that name files made paths from here.
    pub(super) fn resolved_command(&self) -> Vec<String> {
        self.command
            .iter()
            .map(|w| {
                let p = self.dir.join(w);
                if p.is_file() {
                    p.to_string_lossy().into_owned()
                } else {
                    w.clone()
                }
            })
            .collect()
    }

    /// The command as one line, for messages.
    pub fn display(&self) -> String {
        shlex::try_join(self.command.iter().map(String::as_str))
            .unwrap_or_else(|_| self.command.join(" "))
    }
}

fn shown_dir(dir: &Path) -> String {
    if dir.as_os_str().is_empty() || dir == Path::new(".") {
        "the current directory".into()
    } else {
        dir.display().to_string()
    }
}

/// A program's reply timeout must be within [0.01, 3600] s.
pub fn check_timeout(timeout_s: f64) -> Result<(), String> {
    if !(timeout_s.is_finite() && (0.01..=3600.0).contains(&timeout_s)) {
        return Err(format!(
            "the strategy timeout {} s is outside [0.01, 3600] s",
            crate::settings::fmt_num(timeout_s)
        ));
    }
    Ok(())
}

/// One of a program's further `files`: a regular file, named relative to `dir`.
pub fn check_file(dir: &Path, name: &str) -> Result<(), String> {
    if !dir.join(name).is_file() {
        return Err(format!(
            "file '{}' is not a file (files are relative to {})",
            crate::text::excerpt(name),
            shown_dir(dir)
        ));
    }
    relative_parts(name)?;
    Ok(())
}

/// A relative file name as the levels it climbs ("..") and the parts below: refused when
/// absolute or climbing after descending.
fn relative_parts(name: &str) -> Result<(usize, Vec<String>), String> {
    use std::path::Component;
    let (mut up, mut parts) = (0usize, Vec::new());
    for c in Path::new(name).components() {
        match c {
            Component::CurDir => {}
            Component::ParentDir if parts.is_empty() => up += 1,
            Component::ParentDir => {
                parts.pop();
            }
            Component::Normal(p) => parts.push(p.to_string_lossy().into_owned()),
            Component::RootDir | Component::Prefix(_) => {
                return Err(format!(
                    "file '{}' is an absolute path (give it relative to the grid file, so that remote workers can receive it)",
                    crate::text::excerpt(name)
                ))
            }
        }
    }
    if parts.is_empty() {
        return Err(format!(
            "file '{}' names no file",
            crate::text::excerpt(name)
        ));
    }
    Ok((up, parts))
}

/// The identity of a program's files: SHA-256 over their names and contents.
fn files_sha256(files: &[(String, Vec<u8>)]) -> String {
    if files.is_empty() {
        return String::new();
    }
    use sha2::{Digest, Sha256};
    let mut h = Sha256::new();
    for (name, bytes) in files {
        h.update(name.as_bytes());
        h.update([0]);
        h.update((bytes.len() as u64).to_le_bytes());
        h.update(bytes);
    }
    format!("{:x}", h.finalize())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn relative_names_keep_their_layout_inside_the_root() {
        // (name, levels up, parts) or the error's words.
        type Want = Result<(usize, &'static [&'static str]), &'static str>;
        let cases: [(&str, Want); 6] = [
            ("a.py", Ok((0, &["a.py"]))),
            ("./lib/b.py", Ok((0, &["lib", "b.py"]))),
            ("../../python/m.py", Ok((2, &["python", "m.py"]))),
            ("lib/../c.py", Ok((0, &["c.py"]))),
            ("/etc/passwd", Err("absolute path")),
            ("..", Err("names no file")),
        ];
        for (name, want) in cases {
            match (relative_parts(name), want) {
                (Ok((up, parts)), Ok((u, p))) => {
                    assert_eq!(up, u, "{name}");
                    assert_eq!(parts, p, "{name}");
                }
                (Err(e), Err(needle)) => assert!(e.contains(needle), "{name}: {e}"),
                (got, want) => panic!("{name}: got {got:?}, want {want:?}"),
            }
        }
    }

    #[test]
    fn a_materialized_program_is_checked_by_hash() {
        let root = std::env::temp_dir().join(format!("fc-mat-{}", std::process::id()));
        let files = vec![
            ("../s/a.py".to_string(), b"print(1)\n".to_vec()),
            ("../python/m.py".to_string(), b"x = 2\n".to_vec()),
        ];
        let sha = files_sha256(&files);
        let command = vec!["python3".to_string(), "../s/a.py".to_string()];
        let p = StrategyProgram::materialize(
            command.clone(),
            vec!["../python/m.py".into()],
            &files,
            &sha,
            1.0,
            &root,
        )
        .unwrap();
        assert!(p.dir.starts_with(&root));
        assert_eq!(
            std::fs::read(p.dir.join("../python/m.py")).unwrap(),
            b"x = 2\n"
        );
        assert_eq!(p.file_names(), vec!["../s/a.py", "../python/m.py"]);
        let damaged = StrategyProgram::materialize(command, vec![], &files, "00", 1.0, &root);
        assert!(damaged.unwrap_err().contains("damaged"));
        // A file named by an absolute path on the coordinator's machine lands in the job's
        // directory, and the command names it there.
        let abs = vec![("/home/me/s.py".to_string(), b"print(3)\n".to_vec())];
        let p = StrategyProgram::materialize(
            vec!["python3".into(), "/home/me/s.py".into()],
            vec![],
            &abs,
            &files_sha256(&abs),
            1.0,
            &root,
        )
        .unwrap();
        let moved = Path::new(&p.command[1]);
        assert!(moved.starts_with(&root), "{moved:?}");
        assert_eq!(std::fs::read(moved).unwrap(), b"print(3)\n");
        let _ = std::fs::remove_dir_all(&root);
    }
}
